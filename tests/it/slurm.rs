//! scripts/slurm_array.sh with stand-in `sbatch`, `sinfo` and `squeue` (a one-node partition of 2
//! CPUs; sbatch runs the array's tasks and then the merge at once, in order, as the dependency
//! would). The real scheduler is exercised by .ci/slurm on a one-node cluster.

use crate::common::*;
use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const SPEC: &str = r#"
name = "tiny"
master_seed = 5
[optimise]
datasets = ["sphere"]
grid = "20x20"
control_nets = ["6x6"]
parameterisations = ["chord_length"]
optimisers = ["ga", "de", "pso"]
repeats = 2
generations = 20
population = 10
[optimise.som]
iterations = 300
"#;

const SBATCH: &str = r#"#!/usr/bin/env bash
# Stand-in sbatch: records its arguments, runs the script now (every task of an array in order).
echo "$*" >>"$STANDIN_LOG"
array="" output="" script=""
while [ $# -gt 0 ]; do
  case "$1" in
    --array) array="$2"; shift 2 ;;
    --output) output="$2"; shift 2 ;;
    --parsable|--kill-on-invalid-dep=*) shift ;;
    --*) shift 2 ;;
    *) script="$1"; shift ;;
  esac
done
id=$(( $(cat "$STANDIN_LOG" | wc -l) + 100 ))
if [ -n "$array" ]; then
  for i in $(seq "${array%-*}" "${array#*-}"); do
    SLURM_JOB_ID="$id" SLURM_ARRAY_TASK_ID="$i" bash "$script" >"${output//%a/$i}" 2>&1
  done
else
  SLURM_JOB_ID="$id" bash "$script" >"$output" 2>&1
fi
echo "$id"
"#;

const SINFO: &str = r#"#!/usr/bin/env bash
# Stand-in sinfo: one node of 2 CPUs in the default partition "local".
case " $* " in
  *" -p "*) echo 2 ;;
  *) echo "2 local*" ;;
esac
"#;

/// Stand-in squeue: no job is queued or running (sbatch ran them all already).
const SQUEUE: &str = "#!/bin/sh\nexit 0\n";

fn stand_ins(c: &Case) -> PathBuf {
    for (name, text) in [("sbatch", SBATCH), ("sinfo", SINFO), ("squeue", SQUEUE)] {
        let p = c.write(&format!("standin/{name}"), text);
        std::fs::set_permissions(&p, std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();
    }
    c.path("standin")
}

/// Runs scripts/slurm_array.sh in the case folder with the stand-ins first on PATH.
fn array(c: &Case, args: &[&str], env: &[(&str, &str)]) -> Output {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("scripts/slurm_array.sh");
    let path = format!("{}:{}", stand_ins(c).display(), std::env::var("PATH").unwrap_or_default());
    let mut cmd = Command::new(script);
    cmd.args(args)
        .current_dir(c.dir.path())
        .env("PATH", path)
        .env("STANDIN_LOG", c.path("sbatch.log"));
    cmd.env("SOMNURBS_BIN", env!("CARGO_BIN_EXE_somnurbs")).env_remove("CPUS");
    // The tiny spec needs no data files; pass the data folder only when there is one.
    match data_dir() {
        d if d.is_dir() => cmd.env("SOMNURBS_DATA", d),
        _ => cmd.env_remove("SOMNURBS_DATA"),
    };
    for (k, v) in env {
        cmd.env(k, v);
    }
    cmd.output().unwrap()
}

fn show(out: &Output) -> String {
    format!(
        "status: {}\nstdout:\n{}\nstderr:\n{}",
        out.status,
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    )
}

#[test]
fn the_array_runs_the_shards_and_merges_into_the_one_machine_tables() {
    let c = Case::new();
    c.write("tiny.toml", SPEC);
    c.ok(&["run", "tiny.toml", "--out", "one"]);
    let out = array(&c, &["tiny.toml", "3"], &[("OUT", "arr")]);
    assert!(out.status.success(), "{}", show(&out));
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(
        said.contains("submitted array 101 (3 shards of tiny.toml") && said.contains("merge 102"),
        "{said}"
    );
    assert!(said.contains("progress: scripts/slurm_array.sh --status"), "{said}");
    // CPUs per task from the partition (2), and the merge runs after every task, whatever its end.
    let log = std::fs::read_to_string(c.path("sbatch.log")).unwrap();
    assert!(log.lines().all(|l| l.contains("--cpus-per-task 2")), "{log}");
    assert!(log.lines().nth(1).unwrap().contains("--dependency afterany:101"), "{log}");
    let compared = same_tables(&c.path("one"), &c.path("arr/merged"));
    assert!(compared >= 5, "{compared} tables");
    let status = array(&c, &["--status", "arr"], &[]);
    assert!(status.status.success(), "{}", show(&status));
    assert!(
        String::from_utf8_lossy(&status.stdout).contains("shard 3/3: exit 0"),
        "{}",
        show(&status)
    );
    // A second submission would merge into the finished folder: refused before submitting.
    let again = array(&c, &["tiny.toml", "3"], &[("OUT", "arr")]);
    assert_eq!(again.status.code(), Some(2), "{}", show(&again));
    assert!(
        String::from_utf8_lossy(&again.stderr).contains("merged already exists"),
        "{}",
        show(&again)
    );
}

#[test]
fn a_failed_shard_fails_the_merge_naming_it_and_a_resubmission_resumes() {
    let c = Case::new();
    c.write("tiny.toml", SPEC);
    let failing = c.write(
        "failing",
        &format!(
            "#!/bin/sh\n[ \"${{SLURM_ARRAY_TASK_ID:-}}\" = 2 ] && exit 3\nexec {} \"$@\"\n",
            env!("CARGO_BIN_EXE_somnurbs")
        ),
    );
    std::fs::set_permissions(&failing, std::os::unix::fs::PermissionsExt::from_mode(0o755))
        .unwrap();
    let out = array(
        &c,
        &["tiny.toml", "3"],
        &[("OUT", "arr"), ("SOMNURBS_BIN", failing.to_str().unwrap())],
    );
    assert!(out.status.success(), "{}", show(&out));
    let merge_log = std::fs::read_to_string(c.path("arr/logs/merge.log")).unwrap();
    assert!(merge_log.contains("merge refused: shard 2/3 failed (exit 3)"), "{merge_log}");
    assert!(!merge_log.contains("shard 1/3") && !merge_log.contains("shard 3/3"), "{merge_log}");
    assert!(!c.path("arr/merged").exists());
    let status = array(&c, &["--status", "arr"], &[]);
    assert_eq!(status.status.code(), Some(1), "{}", show(&status));
    assert!(
        String::from_utf8_lossy(&status.stdout).contains("merge: failed: shard 2/3 failed"),
        "{}",
        show(&status)
    );
    // The same command again (the shard no longer fails) resumes and merges.
    let out = array(&c, &["tiny.toml", "3"], &[("OUT", "arr")]);
    assert!(out.status.success(), "{}", show(&out));
    assert!(
        c.path("arr/merged/manifest.toml").exists(),
        "{}",
        std::fs::read_to_string(c.path("arr/logs/merge.log")).unwrap_or_default()
    );
}

#[test]
fn a_request_no_node_can_hold_and_bad_arguments_are_refused_before_submitting() {
    let c = Case::new();
    c.write("tiny.toml", SPEC);
    let out = array(&c, &["tiny.toml", "3"], &[("OUT", "arr"), ("CPUS", "4")]);
    assert_eq!(out.status.code(), Some(2), "{}", show(&out));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("CPUS=4 but the largest node in partition (default) has 2 CPUs"), "{err}");
    let out = array(&c, &["tiny.toml", "3", "--profile", "nope"], &[("OUT", "arr")]);
    assert_eq!(out.status.code(), Some(2), "{}", show(&out));
    assert!(String::from_utf8_lossy(&out.stderr).contains("no profile `nope`"), "{}", show(&out));
    let out = array(&c, &["tiny.toml", "3", "--out", "x"], &[]);
    assert_eq!(out.status.code(), Some(2), "{}", show(&out));
    assert!(!c.path("sbatch.log").exists(), "nothing may be submitted");
    assert!(!c.path("arr").exists() && !c.path("results").exists(), "nothing may be written");
}
