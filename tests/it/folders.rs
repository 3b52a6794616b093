//! Issue 35: the folder contract. A result folder holds one run (or one plan), whole, and nothing
//! else: a writer refuses a folder holding anything else, naming what is there; the manifest is
//! the last write; `--resume` removes its own leftovers; single-file writers stay out of result
//! folders and replace only regular files; a tiny run never waits a progress interval.

use crate::common::*;
use std::time::{Duration, Instant};

/// A SOM spec of a fraction of a second.
fn som() -> String {
    SOM_TINY.replace("DATA", "sphere")
}

#[test]
fn a_finished_folder_is_never_mixed_with_another_run() {
    let c = Case::new();
    c.write("a.toml", &som());
    c.write("other.toml", &SPEC.replace("name = \"d\"", "name = \"s\""));
    c.ok(&["run", "a.toml", "--out", "o"]);
    let before = snapshot(&c.path("o"));
    assert!(before.iter().any(|(f, _)| f == "manifest.toml"));
    // Another spec of the same name, the same spec again, the same through a link: all refused.
    c.fails(
        &["run", "other.toml", "--out", "o"],
        &["o", "already holds a finished run of spec `s`"],
    );
    c.fails(&["run", "a.toml", "--out", "o"], &["already holds a finished run"]);
    std::os::unix::fs::symlink(c.path("o"), c.path("link")).unwrap();
    c.fails(&["run", "other.toml", "--out", "link"], &["already holds a finished run"]);
    // --resume of another run is refused naming the difference; of this run, nothing to do.
    c.fails(&["run", "other.toml", "--out", "o", "--resume"], &["cannot resume", "different run"]);
    let out = c.ok(&["run", "a.toml", "--out", "o", "--resume"]);
    assert!(String::from_utf8_lossy(&out.stderr).contains("nothing to do"));
    // fit and merge into it, and a folder of someone else's files: refused, naming what is there.
    c.write("g.csv", &crate::robust::small_grid(6));
    c.fails(&["fit", "--grid", "g.csv", "--cn", "4x4", "--out", "o"], &["already holds"]);
    c.fails(&["merge", "x", "--out", "o"], &["merge", "already holds"]);
    c.write("afile", "mine\n");
    c.fails(&["run", "a.toml", "--out", "afile"], &["afile", "is not a folder"]);
    c.write("mine/notes.txt", "mine\n");
    c.fails(&["run", "a.toml", "--out", "mine"], &["mine", "not a somnurbs result", "notes.txt"]);
    assert_eq!(std::fs::read_to_string(c.path("mine/notes.txt")).unwrap(), "mine\n");
    assert!(snapshot(&c.path("o")) == before, "the finished folder changed");
}

#[test]
fn a_sweep_folder_is_not_rerun_without_its_sweep() {
    let c = Case::new();
    c.write("s.toml", SPEC);
    c.ok(&["run", "s.toml", "--out", "sw", "--sweep", "optimise.de.f=0.3,0.5"]);
    let before = snapshot(&c.path("sw"));
    c.fails(&["run", "s.toml", "--out", "sw"], &["already holds a finished run of spec `d`"]);
    c.fails(&["run", "s.toml", "--out", "sw", "--resume"], &["cannot resume", "different run"]);
    assert!(snapshot(&c.path("sw")) == before, "the sweep's folder changed");
}

#[test]
fn the_manifest_is_the_last_write_and_resume_cleans_its_leftovers() {
    let c = Case::new();
    c.write("s.toml", SPEC);
    c.ok(&["run", "s.toml", "--out", "o"]);
    // What a kill just before the manifest leaves, with temporary files of the interrupted writes.
    std::fs::remove_file(c.path("o/manifest.toml")).unwrap();
    c.write("o/.runs.csv.4242.7.tmp", "half a table");
    c.write("o/png/.x.png.4242.8.tmp", "half a picture");
    std::fs::create_dir_all(c.path("o/.compare.4242.9.staged/png")).unwrap();
    // The page cannot be written (a folder sits where report.html goes): the run fails, and the
    // folder is still unfinished, with no manifest.
    std::fs::remove_file(c.path("o/report.html")).unwrap();
    c.write("o/report.html/x", "");
    let out = c.run(&["run", "s.toml", "--out", "o", "--resume"]);
    let err = String::from_utf8_lossy(&out.stderr).to_string();
    assert!(
        out.status.code() == Some(2) && err.contains("report.html") && err.contains("a folder"),
        "{err}"
    );
    assert!(!c.path("o/manifest.toml").exists(), "a manifest beside a page that failed");
    c.fails(&["drift", "o", "o"], &["unfinished"]);
    std::fs::remove_dir_all(c.path("o/report.html")).unwrap();
    c.ok(&["run", "s.toml", "--out", "o", "--resume"]);
    assert!(c.path("o/manifest.toml").exists() && c.path("o/report.html").is_file());
    let left: Vec<String> = walk(&c.path("o"))
        .iter()
        .map(|p| p.display().to_string())
        .filter(|p| p.contains(".4242."))
        .collect();
    assert!(left.is_empty(), "leftovers after --resume: {left:?}");
    assert!(!c.path("o/.compare.4242.9.staged").exists());
}

#[test]
fn a_plan_folder_holds_exactly_its_plan() {
    let c = Case::new();
    c.write("specs/a.toml", &SPEC.replace("name = \"d\"", "name = \"a\""));
    c.write("specs/b.toml", &som().replace("name = \"s\"", "name = \"b\""));
    c.write("specs/p.toml", "title = \"two\"\nspecs = [\"a\", \"b\"]\n");
    c.write("specs/short.toml", "title = \"one\"\nspecs = [\"a\"]\n");
    let run = |plan: &str, resume: bool| -> Vec<String> {
        let mut args = vec![
            "reproduce",
            "--plan",
            plan,
            "--specs",
            "specs",
            "--profile",
            "quick",
            "--out",
            "p",
        ];
        if resume {
            args.push("--resume");
        }
        args.into_iter().map(String::from).collect()
    };
    c.ok(&strs(&run("p", false)));
    assert!(
        c.path("p/plan_fingerprint.toml").exists() && !c.path("p/.somnurbs-incomplete").exists()
    );
    let before = snapshot(&c.path("p"));
    c.fails(&strs(&run("p", false)), &["already holds a finished reproduction"]);
    c.fails(&strs(&run("short", false)), &["already holds a finished reproduction"]);
    c.fails(
        &strs(&run("short", true)),
        &["cannot resume", "another reproduction", "plan: p vs short"],
    );
    let out = c.ok(&strs(&run("p", true)));
    assert!(String::from_utf8_lossy(&out.stderr).contains("nothing to do"));
    assert!(snapshot(&c.path("p")) == before, "the finished plan folder changed");
    // An interrupted reproduction resumes: its finished spec folders stay as they are; a folder
    // the plan does not make is refused.
    std::fs::write(c.path("p/.somnurbs-incomplete"), "").unwrap();
    std::fs::create_dir(c.path("p/old_spec")).unwrap();
    c.fails(&strs(&run("p", true)), &["cannot resume", "p/old_spec", "not one of this plan's"]);
    std::fs::remove_dir(c.path("p/old_spec")).unwrap();
    std::fs::remove_file(c.path("p/b/manifest.toml")).unwrap();
    let a_before = snapshot(&c.path("p/a"));
    c.ok(&strs(&run("p", true)));
    assert!(snapshot(&c.path("p/a")) == a_before, "a finished spec folder was rewritten");
    assert!(c.path("p/b/manifest.toml").exists() && !c.path("p/.somnurbs-incomplete").exists());
}

#[test]
fn single_file_writers_stay_out_of_result_folders_and_replace_only_regular_files() {
    let c = Case::new();
    c.write("s.toml", SPEC);
    c.ok(&["run", "s.toml", "--out", "o"]);
    let before = snapshot(&c.path("o"));
    c.fails(&["datasets", "export", "sphere", "o/runs.csv"], &["inside the result folder", "o"]);
    c.fails(&["datasets", "export", "sphere", "o/png/new.xyz"], &["inside the result folder"]);
    c.fails(&["drift", "o", "o", "--out", "o/drift.csv"], &["inside the result folder"]);
    assert!(snapshot(&c.path("o")) == before, "the finished folder changed");
    // drift writes its CSV in the working folder by default, not into the run.
    c.ok(&["drift", "o", "o"]);
    assert!(c.path("drift.csv").exists() && !c.path("o/drift.csv").exists());
    // A named pipe and a link are not replaced by a regular file.
    let fifo = c.path("pipe.xyz");
    let status = std::process::Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(status.success());
    c.fails(&["datasets", "export", "sphere", "pipe.xyz"], &["pipe.xyz", "named pipe"]);
    use std::os::unix::fs::FileTypeExt;
    assert!(std::fs::symlink_metadata(&fifo).unwrap().file_type().is_fifo());
    c.write("target.xyz", "keep\n");
    std::os::unix::fs::symlink(c.path("target.xyz"), c.path("link.xyz")).unwrap();
    c.fails(&["datasets", "export", "sphere", "link.xyz"], &["symbolic link"]);
    assert_eq!(std::fs::read_to_string(c.path("target.xyz")).unwrap(), "keep\n");
    c.ok(&["datasets", "export", "sphere", "plain.xyz"]);
    c.ok(&["datasets", "export", "sphere", "plain.xyz"]);
}

#[test]
fn compare_writes_a_folder_of_its_own_and_leaves_the_run_as_it_was() {
    let c = Case::new();
    let spec = SPEC
        .replace("repeats = 2", "repeats = 3")
        .replace("control_nets = [\"6x6\"]", "control_nets = [\"6x6\", \"8x8\"]");
    c.write("s.toml", &spec);
    c.ok(&["run", "s.toml", "--out", "o"]);
    let run_files = snapshot(&c.path("o"));
    c.ok(&["compare", "o", "--bayes-samples", "1000"]);
    let (_, rows) = read_csv(&c.path("o/compare/compare_cells.csv"));
    assert_eq!(rows.len(), 2);
    assert!(c.path("o/compare/compare.toml").exists());
    let without_compare: Vec<(String, Vec<u8>)> =
        snapshot(&c.path("o")).into_iter().filter(|(f, _)| !f.starts_with("compare/")).collect();
    assert!(without_compare == run_files, "compare changed the run's own files");
    // A second compare replaces its folder whole; a foreign --out is refused.
    c.write("o/compare/stale.csv", "x\n1\n");
    c.ok(&["compare", "o", "--bayes-samples", "1000"]);
    assert!(!c.path("o/compare/stale.csv").exists());
    c.write("elsewhere/keep.txt", "k\n");
    c.fails(&["compare", "o", "--out", "elsewhere"], &["elsewhere", "keep.txt"]);
    c.ok(&["compare", "o", "--out", "fresh", "--bayes-samples", "1000"]);
    assert!(c.path("fresh/compare_overall.csv").exists());
    // An unfinished run is not compared.
    std::fs::remove_file(c.path("o/manifest.toml")).unwrap();
    c.fails(&["compare", "o"], &["unfinished"]);
}

#[test]
fn a_tiny_run_never_waits_a_progress_interval() {
    let c = Case::new();
    c.write("a.toml", &som());
    // The default interval is 15 s; the runs' stderr is a pipe, so the plain progress lines run.
    for k in 0..12 {
        let out_dir = format!("o{k}");
        let t0 = Instant::now();
        let out = bin()
            .args(["run", "a.toml", "--out", &out_dir, "--jobs", "2"])
            .current_dir(c.dir.path())
            .env_remove("SOMNURBS_PROGRESS_SECS")
            .output()
            .unwrap();
        assert!(out.status.success(), "{}", c.explain(&["run", "a.toml"], &out));
        let took = t0.elapsed();
        assert!(took < Duration::from_secs(5), "run {k} took {took:?}: a missed stop");
    }
}

fn strs(v: &[String]) -> Vec<&str> {
    v.iter().map(String::as_str).collect()
}
